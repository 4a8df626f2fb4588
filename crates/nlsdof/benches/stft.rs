//! STFT spectrogram benchmark: `cargo bench -p nlsdof --bench stft`.
//!
//! The paper's longest record, 8 752 000 samples at 2048 Hz, with its
//! section 4.5 settings: symmetric Hamming, L = ⌊N/15⌋ = 583 466, 50 %
//! overlap → 29 segments, 291 734 one-sided bins (8.46 M values). Issue 6
//! target: ≤ 1 s.
//!
//! `583 466 = 2 · 13 · 22 441`: realfft turns the even-length real FFT into
//! a complex FFT of `291 733 = 13 · 22 441`; rustfft's AVX planner does the
//! prime 22 441 by Bluestein's algorithm (callgrind: `BluesteinsAvx` over
//! `MixedRadix6xnAvx`/`MixedRadix9xnAvx` inner FFTs). Cases:
//!
//! 1. default (`nfft = L`, scipy's `nfft = nperseg`), rayon's default pool;
//! 2. the same on one thread (the parallel speed-up);
//! 3. zero-padded to `next_fast_len(L) = 588 000 = 2⁵·3·5³·7²` (a
//!    different bin grid; shown for comparison only, not the default);
//! 4. building the FFT plan alone (paid once per call);
//! 5. the Eq 33 comparison of two such spectrograms.
//!
//! `NLSDOF_BENCH=once` runs a single spectrogram instead (for callgrind
//! instruction counts or `perf stat` on a busy machine).
//!
//! The signal: a phase-continuous stepped sine over 5.3–5.5 Hz (200 steps)
//! plus 2 % pseudo-random noise.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use nlsdof::signal_processing::stft::{compare, next_fast_len, spectrogram, StftOptions};
use std::f64::consts::TAU;
use std::time::Duration;

const N: usize = 8_752_000;
const FS: f64 = 2048.0;

fn signal(seed: u64, gain: f64) -> Vec<f64> {
    let mut state = seed;
    let mut phase = 0.0;
    let per_step = N / 200;
    (0..N)
        .map(|i| {
            let f = 5.3 + 0.2 * (i / per_step).min(199) as f64 / 199.0;
            phase += TAU * f / FS;
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let noise = ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0;
            gain * 0.62 * phase.sin() + 0.02 * 0.62 * noise
        })
        .collect()
}

/// `NLSDOF_BENCH=once`: one spectrogram of the full record (default
/// options, rayon's default pool) and its wall time, for instruction counts
/// (`valgrind --tool=callgrind`) or `perf stat` without criterion's loop.
fn once() {
    let x = signal(1, 1.0);
    let paper = StftOptions::paper(N, FS);
    let t = std::time::Instant::now();
    let s = spectrogram(black_box(&x), &paper).unwrap();
    eprintln!(
        "one spectrogram: {} x {} in {:.3} s (rayon threads: {})",
        s.n_time,
        s.n_freq,
        t.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
}

fn bench(c: &mut Criterion) {
    if std::env::var("NLSDOF_BENCH").as_deref() == Ok("once") {
        once();
        return;
    }
    let x = signal(1, 1.0);
    let paper = StftOptions::paper(N, FS);
    let lay = paper.layout(N).unwrap();
    eprintln!(
        "N = {N}, L = {}, hop = {}, segments = {}, bins = {}, next_fast_len(L) = {}, rayon threads = {}",
        lay.segment_len,
        lay.hop,
        lay.n_segments,
        lay.n_freq,
        next_fast_len(lay.segment_len),
        rayon::current_num_threads()
    );
    let mut g = c.benchmark_group("stft");
    g.sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(8));
    g.bench_function("8752000 samples, L=N/15, 50% overlap, nfft=L", |b| {
        b.iter(|| spectrogram(black_box(&x), &paper).unwrap())
    });
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    g.bench_function("same, 1 thread", |b| {
        b.iter(|| one.install(|| spectrogram(black_box(&x), &paper).unwrap()))
    });
    let mut padded = paper;
    padded.nfft = Some(next_fast_len(lay.segment_len));
    g.bench_function("same, nfft=next_fast_len(L) (zero-padded)", |b| {
        b.iter(|| spectrogram(black_box(&x), &padded).unwrap())
    });
    g.bench_function("realfft plan only, length 583466", |b| {
        b.iter(|| realfft::RealFftPlanner::<f64>::new().plan_fft_forward(black_box(583_466)))
    });
    let a = spectrogram(&x, &paper).unwrap();
    let m = spectrogram(&signal(2, 1.01), &paper).unwrap();
    g.bench_function(
        "compare (Eq 33 + robust) of two 29 x 291734 spectrograms",
        |b| b.iter(|| compare(black_box(&a), black_box(&m), 0.01).unwrap()),
    );
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
