//! STFT spectrograms and the Eq 33 comparison (paper section 4.5).
//!
//! Oracles: scipy.signal.spectrogram reference values
//! (tests/data/stft_reference.txt, written by scripts/stft_reference.py), a
//! naive O(L²) DFT of each segment written out from the definition, the
//! analytic amplitude of a pure tone, and Parseval's identity.

use nlsdof::signal_processing::stft::{
    compare, next_fast_len, spectrogram, Detrend, Scaling, Spectrogram, StftError, StftOptions,
};
use nlsdof::signal_processing::{Symmetry, Window};
use std::f64::consts::PI;

/// Deterministic pseudo-random numbers in [-1, 1) (64-bit LCG, top bits).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

#[allow(clippy::too_many_arguments)]
fn opts(
    window: Window,
    symmetry: Symmetry,
    l: usize,
    overlap: f64,
    nfft: Option<usize>,
    fs: f64,
    detrend: Detrend,
    scaling: Scaling,
) -> StftOptions {
    StftOptions {
        window,
        symmetry,
        segment_len: l,
        overlap,
        nfft,
        sample_rate: fs,
        detrend,
        scaling,
    }
}

// ---------------------------------------------------------------- scipy

struct Case {
    name: String,
    window: Window,
    symmetry: Symmetry,
    l: usize,
    noverlap: usize,
    nfft: usize,
    detrend: Detrend,
    magnitude_mode: bool,
    freqs: Vec<f64>,
    times: Vec<f64>,
    n_time: usize,
    n_freq: usize,
    values: Vec<f64>,
}

fn load_reference() -> (f64, Vec<f64>, Vec<Case>) {
    let text = include_str!("data/stft_reference.txt");
    let toks: Vec<&str> = text
        .lines()
        .filter(|l| !l.trim_start().starts_with('#'))
        .flat_map(|l| l.split_whitespace())
        .collect();
    let mut pos = 0usize;
    let mut next = || {
        pos += 1;
        *toks.get(pos - 1).expect("reference file truncated")
    };
    let num = |s: &str| s.parse::<f64>().unwrap();
    assert_eq!(next(), "fs");
    let fs = num(next());
    assert_eq!(next(), "signal");
    let n: usize = next().parse().unwrap();
    let x: Vec<f64> = (0..n).map(|_| num(next())).collect();
    let mut cases = Vec::new();
    let n_cases = text.lines().filter(|l| l.starts_with("case ")).count();
    for _ in 0..n_cases {
        assert_eq!(next(), "case");
        let name = next().to_string();
        let mut kv = std::collections::HashMap::new();
        for _ in 0..7 {
            let k = next().to_string();
            kv.insert(k, next().to_string());
        }
        let window = match kv["window"].as_str() {
            "hamming" => Window::Hamming,
            "hann" => Window::Hann,
            "blackman" => Window::Blackman,
            "rectangular" => Window::Rectangular,
            w => panic!("window {w}"),
        };
        let symmetry = match kv["symmetry"].as_str() {
            "symmetric" => Symmetry::Symmetric,
            _ => Symmetry::Periodic,
        };
        assert_eq!(next(), "freqs");
        let nf: usize = next().parse().unwrap();
        let freqs = (0..nf).map(|_| num(next())).collect();
        assert_eq!(next(), "times");
        let nt: usize = next().parse().unwrap();
        let times = (0..nt).map(|_| num(next())).collect();
        assert_eq!(next(), "values");
        let n_time: usize = next().parse().unwrap();
        let n_freq: usize = next().parse().unwrap();
        let values = (0..n_time * n_freq).map(|_| num(next())).collect();
        assert_eq!(next(), "end");
        cases.push(Case {
            name,
            window,
            symmetry,
            l: kv["L"].parse().unwrap(),
            noverlap: kv["noverlap"].parse().unwrap(),
            nfft: kv["nfft"].parse().unwrap(),
            detrend: if kv["detrend"] == "constant" {
                Detrend::Constant
            } else {
                Detrend::None
            },
            magnitude_mode: kv["mode"] == "magnitude",
            freqs,
            times,
            n_time,
            n_freq,
            values,
        });
    }
    (fs, x, cases)
}

#[test]
fn matches_scipy_spectrogram() {
    let (fs, x, cases) = load_reference();
    assert_eq!(cases.len(), 4);
    for c in &cases {
        let scaling = if c.magnitude_mode {
            Scaling::Amplitude
        } else {
            Scaling::Psd
        };
        let o = opts(
            c.window,
            c.symmetry,
            c.l,
            c.noverlap as f64 / c.l as f64,
            Some(c.nfft),
            fs,
            c.detrend,
            scaling,
        );
        let lay = o.layout(x.len()).unwrap();
        assert_eq!(lay.noverlap, c.noverlap, "{}", c.name);
        let s = spectrogram(&x, &o).unwrap();
        assert_eq!((s.n_time, s.n_freq), (c.n_time, c.n_freq), "{}", c.name);
        for (a, b) in s.frequencies.iter().zip(&c.freqs) {
            assert!(
                (a - b).abs() <= 1e-12 * b.abs().max(1.0),
                "{}: f {a} vs {b}",
                c.name
            );
        }
        for (a, b) in s.times.iter().zip(&c.times) {
            assert!(
                (a - b).abs() <= 1e-12 * b.abs().max(1.0),
                "{}: t {a} vs {b}",
                c.name
            );
        }
        let peak = c.values.iter().fold(0.0f64, |m, v| m.max(*v));
        let nyquist = if c.nfft % 2 == 0 {
            Some(c.nfft / 2)
        } else {
            None
        };
        for t in 0..c.n_time {
            for k in 0..c.n_freq {
                let mut want = c.values[t * c.n_freq + k];
                if c.magnitude_mode && k != 0 && Some(k) != nyquist {
                    // Scaling::Amplitude = scipy 'magnitude'/'spectrum' × c_k (c_k = 2 off DC/Nyquist)
                    want *= 2.0;
                }
                let got = s.at(t, k);
                assert!(
                    (got - want).abs() <= 1e-12 * peak,
                    "{}: segment {t} bin {k}: {got} vs scipy {want}",
                    c.name
                );
            }
        }
    }
}

// ---------------------------------------------------------------- naive DFT oracle

/// The spectrogram straight from the definition: per segment, an O(L·N_fft)
/// DFT with explicitly evaluated twiddles (angles reduced mod N_fft exactly
/// in integers), windowing and scaling written out independently.
fn naive_spectrogram(x: &[f64], o: &StftOptions) -> Vec<Vec<f64>> {
    let l = o.segment_len;
    let nfft = o.nfft.unwrap_or(l);
    let noverlap = ((o.overlap * l as f64).round() as usize).min(l - 1);
    let hop = l - noverlap;
    let m = 1 + (x.len() - l) / hop;
    let w = o.window.coefficients(l, o.symmetry);
    let sw: f64 = w.iter().sum();
    let sw2: f64 = w.iter().map(|v| v * v).sum();
    (0..m)
        .map(|seg| {
            let xs = &x[seg * hop..seg * hop + l];
            let mu = if o.detrend == Detrend::Constant {
                xs.iter().sum::<f64>() / l as f64
            } else {
                0.0
            };
            (0..=nfft / 2)
                .map(|k| {
                    let (mut re, mut im) = (0.0, 0.0);
                    for n in 0..l {
                        let ang = -2.0 * PI * ((k * n) % nfft) as f64 / nfft as f64;
                        let y = w[n] * (xs[n] - mu);
                        re += y * ang.cos();
                        im += y * ang.sin();
                    }
                    let p = re * re + im * im;
                    let c = if k == 0 || 2 * k == nfft { 1.0 } else { 2.0 };
                    match o.scaling {
                        Scaling::Amplitude => c * p.sqrt() / sw,
                        Scaling::Psd => c * p / (o.sample_rate * sw2),
                    }
                })
                .collect()
        })
        .collect()
}

#[test]
fn fft_path_matches_naive_dft() {
    let mut rng = Lcg(7);
    let x: Vec<f64> = (0..2000).map(|_| rng.next() + 0.3).collect();
    // Lengths exercising realfft's even path with awkward halves (2·37, 2·13·17),
    // odd primes (97), a mixed odd length (7·11·13 = 1001), powers of two and padding.
    let configs = [
        (
            74,
            0.5,
            None,
            Window::Hamming,
            Symmetry::Symmetric,
            Detrend::None,
            Scaling::Amplitude,
        ),
        (
            442,
            0.5,
            None,
            Window::Hann,
            Symmetry::Periodic,
            Detrend::Constant,
            Scaling::Psd,
        ),
        (
            97,
            0.3,
            None,
            Window::Blackman,
            Symmetry::Symmetric,
            Detrend::None,
            Scaling::Psd,
        ),
        (
            1001,
            0.5,
            None,
            Window::Rectangular,
            Symmetry::Symmetric,
            Detrend::Constant,
            Scaling::Amplitude,
        ),
        (
            128,
            0.75,
            None,
            Window::Hamming,
            Symmetry::Periodic,
            Detrend::None,
            Scaling::Amplitude,
        ),
        (
            100,
            0.0,
            Some(131),
            Window::Hann,
            Symmetry::Symmetric,
            Detrend::None,
            Scaling::Psd,
        ),
        (
            50,
            0.5,
            Some(next_fast_len(101)),
            Window::Hamming,
            Symmetry::Symmetric,
            Detrend::Constant,
            Scaling::Amplitude,
        ),
    ];
    for (l, ov, nfft, win, sym, det, sc) in configs {
        let o = opts(win, sym, l, ov, nfft, 512.0, det, sc);
        let s = spectrogram(&x, &o).unwrap();
        let r = naive_spectrogram(&x, &o);
        assert_eq!(s.n_time, r.len());
        let peak = s.max();
        for (t, row) in r.iter().enumerate() {
            assert_eq!(row.len(), s.n_freq);
            for (k, &want) in row.iter().enumerate() {
                let got = s.at(t, k);
                assert!(
                    (got - want).abs() <= 1e-11 * peak,
                    "L={l} nfft={nfft:?}: segment {t} bin {k}: fft {got} vs dft {want}"
                );
            }
        }
    }
}

// ---------------------------------------------------------------- tone, Parseval

#[test]
fn pure_tone_lands_in_its_bin_with_its_amplitude() {
    // N = 15 000 samples at 1 kHz: paper L = 1000, bins every 1 Hz.
    let fs = 1000.0;
    let (amp, f0, phase) = (2.5, 123.0, 0.7);
    let x: Vec<f64> = (0..15_000)
        .map(|n| amp * (2.0 * PI * f0 * n as f64 / fs + phase).sin())
        .collect();
    for (win, sym) in [
        (Window::Hamming, Symmetry::Symmetric),
        (Window::Hann, Symmetry::Periodic),
        (Window::Blackman, Symmetry::Symmetric),
        (Window::Rectangular, Symmetry::Symmetric),
    ] {
        let mut o = StftOptions::paper(x.len(), fs);
        o.window = win;
        o.symmetry = sym;
        let s = spectrogram(&x, &o).unwrap();
        assert_eq!(s.n_freq, 501);
        assert_eq!(s.n_time, 29);
        assert_eq!(s.frequencies[123], 123.0);
        for t in 0..s.n_time {
            let row = s.row(t);
            let kmax = (0..row.len())
                .max_by(|&a, &b| row[a].total_cmp(&row[b]))
                .unwrap();
            assert_eq!(kmax, 123, "{win:?}");
            // Mirror-image leakage from -f0 (246 bins away) is below 1e-4 A.
            assert!(
                (row[123] - amp).abs() < 1e-4 * amp,
                "{win:?}: {} vs {amp}",
                row[123]
            );
        }
        // PSD: the integrated density is the mean square A²/2.
        o.scaling = Scaling::Psd;
        let p = spectrogram(&x, &o).unwrap();
        let df = fs / 1000.0;
        let ms: f64 = p.row(3).iter().sum::<f64>() * df;
        assert!(
            (ms - amp * amp / 2.0).abs() < 1e-3 * amp * amp,
            "{win:?}: {ms}"
        );
    }
}

#[test]
fn parseval_per_segment() {
    // One-sided form of Σ_{k<N_fft} |X_k|² = N_fft Σ_n y_n², y_n = w_n (x_n − μ):
    //   Psd:        Σ_k s_k · f_s/N_fft   = Σ_n y_n² / Σ_n w_n²
    //   Amplitude:  Σ_k s_k² / c_k · (Σw)² = N_fft Σ_n y_n²
    let mut rng = Lcg(99);
    let fs = 200.0;
    let x: Vec<f64> = (0..3000).map(|_| rng.next() * 3.0 + 1.0).collect();
    for (l, nfft, det) in [
        (200, None, Detrend::None),
        (201, None, Detrend::Constant),
        (150, Some(256), Detrend::None),
        (150, Some(255), Detrend::Constant),
    ] {
        let mut o = opts(
            Window::Hamming,
            Symmetry::Symmetric,
            l,
            0.5,
            nfft,
            fs,
            det,
            Scaling::Psd,
        );
        let lay = o.layout(x.len()).unwrap();
        let nf = lay.nfft;
        let w = Window::Hamming.coefficients(l, Symmetry::Symmetric);
        let sw: f64 = w.iter().sum();
        let sw2: f64 = w.iter().map(|v| v * v).sum();
        let psd = spectrogram(&x, &o).unwrap();
        o.scaling = Scaling::Amplitude;
        let amp = spectrogram(&x, &o).unwrap();
        for m in 0..psd.n_time {
            let seg = &x[m * lay.hop..m * lay.hop + l];
            let mu = if det == Detrend::Constant {
                seg.iter().sum::<f64>() / l as f64
            } else {
                0.0
            };
            let energy: f64 = seg
                .iter()
                .zip(&w)
                .map(|(v, wn)| (wn * (v - mu)).powi(2))
                .sum();
            let lhs: f64 = psd.row(m).iter().sum::<f64>() * fs / nf as f64;
            assert!((lhs - energy / sw2).abs() < 1e-12 * energy / sw2, "L={l}");
            let lhs2: f64 = amp
                .row(m)
                .iter()
                .enumerate()
                .map(|(k, s)| {
                    let c = if k == 0 || 2 * k == nf { 1.0 } else { 2.0 };
                    s * s / c
                })
                .sum::<f64>()
                * sw
                * sw;
            assert!(
                (lhs2 - nf as f64 * energy).abs() < 1e-12 * nf as f64 * energy,
                "L={l}"
            );
        }
    }
}

#[test]
fn layout_of_the_paper_record_and_thread_independence() {
    // 8 752 000 samples, L = N/15: 29 segments of 583 466 hopping by 291 733.
    let o = StftOptions::paper(8_752_000, 2048.0);
    let lay = o.layout(8_752_000).unwrap();
    assert_eq!(lay.segment_len, 583_466);
    assert_eq!((lay.noverlap, lay.hop), (291_733, 291_733));
    assert_eq!(lay.n_segments, 29);
    assert_eq!(lay.n_freq, 291_734);
    assert_eq!(lay.used_samples, 8_751_990);

    // Bit-identical results on 1 and 2 threads.
    let mut rng = Lcg(3);
    let x: Vec<f64> = (0..60_000).map(|_| rng.next()).collect();
    let o = StftOptions::with_segments(x.len(), 1000.0, 20);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| spectrogram(&x, &o).unwrap());
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
        .install(|| spectrogram(&x, &o).unwrap());
    assert!(one
        .magnitude
        .iter()
        .zip(&two.magnitude)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
}

#[test]
fn detrend_constant_removes_an_offset() {
    let fs = 100.0;
    let tone: Vec<f64> = (0..3000)
        .map(|n| (2.0 * PI * 7.0 * n as f64 / fs).sin())
        .collect();
    let shifted: Vec<f64> = tone.iter().map(|v| v + 5.0).collect();
    let mut o = StftOptions::paper(tone.len(), fs);
    o.detrend = Detrend::Constant;
    let a = spectrogram(&tone, &o).unwrap();
    let b = spectrogram(&shifted, &o).unwrap();
    for (p, q) in a.magnitude.iter().zip(&b.magnitude) {
        assert!((p - q).abs() < 1e-12);
    }
    // Without detrending the offset shows at DC: 5 (amplitude scaling, c_0 = 1).
    o.detrend = Detrend::None;
    let c = spectrogram(&shifted, &o).unwrap();
    assert!((c.at(0, 0) - 5.0).abs() < 0.01, "{}", c.at(0, 0));
}

// ---------------------------------------------------------------- Eq 33

#[test]
fn eq33_blows_up_on_near_zero_bins_the_robust_variant_does_not() {
    // "Measured" and "model": the same 5 Hz response, the model 1 % too
    // large, each with its own tiny noise floor (1e-6 of the amplitude:
    // sensor noise / integration round-off). Where there is signal the
    // model is 1 % off; Eq 33 instead reports the ratio of two unrelated
    // noise values in some empty bin.
    let fs = 100.0;
    let n = 30_000;
    let mut r1 = Lcg(11);
    let mut r2 = Lcg(12);
    let clean: Vec<f64> = (0..n)
        .map(|i| (2.0 * PI * 5.0 * i as f64 / fs).sin())
        .collect();
    let measured: Vec<f64> = clean.iter().map(|v| v + 1e-6 * r1.next()).collect();
    let model: Vec<f64> = clean.iter().map(|v| 1.01 * v + 1e-6 * r2.next()).collect();
    let o = StftOptions::paper(n, fs);
    let se = spectrogram(&measured, &o).unwrap();
    let sn = spectrogram(&model, &o).unwrap();
    let d = compare(&se, &sn, 0.01).unwrap();
    assert!(
        d.max_relative_percent > 100.0,
        "Eq 33 = {} %",
        d.max_relative_percent
    );
    assert!(
        (d.robust_max_relative_percent - 1.0).abs() < 0.01,
        "robust = {} %",
        d.robust_max_relative_percent
    );
    assert!((d.robust_at_frequency - 5.0).abs() < 0.1);
    assert!(d.bins_compared > 0 && d.bins_compared < d.bins_total / 10);
    assert_eq!(d.bins_total, se.n_time * se.n_freq);
    assert!((d.global_relative_percent - 1.0).abs() < 0.01);
    // Without the noise floors Eq 33 is the 1 % everywhere (the STFT is
    // linear), up to round-off: far sidelobe bins are ~1e-9 of the peak, where
    // an FFT error of ~1e-16 of the peak is ~1e-7 relative (1e-5 %).
    let model_clean: Vec<f64> = clean.iter().map(|v| 1.01 * v).collect();
    let sc = spectrogram(&clean, &o).unwrap();
    let smc = spectrogram(&model_clean, &o).unwrap();
    let d0 = compare(&sc, &smc, 0.0).unwrap();
    assert!(
        (d0.max_relative_percent - 1.0).abs() < 1e-4,
        "{}",
        d0.max_relative_percent
    );
    assert_eq!(d0.robust_max_relative_percent, d0.max_relative_percent);
    assert_eq!(d0.bins_compared, d0.bins_total);
    println!(
        "Eq 33 = {:.4e} % at {:.2} s, {:.3} Hz; robust (floor {}) = {:.4} % at {:.3} Hz over {}/{} bins",
        d.max_relative_percent,
        d.at_time,
        d.at_frequency,
        d.floor_fraction,
        d.robust_max_relative_percent,
        d.robust_at_frequency,
        d.bins_compared,
        d.bins_total
    );
}

#[test]
fn eq33_uses_the_absolute_difference_and_handles_zero_bins() {
    let mk = |v: Vec<f64>| Spectrogram {
        frequencies: vec![0.0, 1.0],
        times: vec![0.5, 1.0],
        magnitude: v,
        n_freq: 2,
        n_time: 2,
        scaling: Scaling::Amplitude,
    };
    let e = mk(vec![1.0, 2.0, 0.0, 4.0]);
    // over-prediction by 50 % at (t=0, k=1) must count
    let s = mk(vec![1.0, 3.0, 0.0, 4.0]);
    let d = compare(&e, &s, 0.0).unwrap();
    assert_eq!(d.max_relative_percent, 50.0);
    assert_eq!((d.at_time, d.at_frequency), (0.5, 1.0));
    // 0 vs 0 is no difference; 0 vs non-zero is an infinite one
    let s2 = mk(vec![1.0, 2.0, 1e-9, 4.0]);
    let d2 = compare(&e, &s2, 0.0).unwrap();
    assert_eq!(d2.max_relative_percent, f64::INFINITY);
    assert_eq!((d2.at_time, d2.at_frequency), (1.0, 0.0));
    let d3 = compare(&e, &s2, 0.1).unwrap();
    assert_eq!(d3.robust_max_relative_percent, 0.0);
    assert_eq!(d3.bins_compared, 3);
}

// ---------------------------------------------------------------- errors

#[test]
fn errors_carry_the_offending_values() {
    let x = vec![0.5; 100];
    let good = StftOptions::with_segments(100, 10.0, 5);
    assert!(spectrogram(&x, &good).is_ok());
    assert_eq!(spectrogram(&[], &good), Err(StftError::Empty));
    let mut y = x.clone();
    y[42] = f64::NAN;
    match spectrogram(&y, &good) {
        Err(StftError::NotFinite { index: 42, value }) => assert!(value.is_nan()),
        other => panic!("{other:?}"),
    }
    y[42] = f64::NEG_INFINITY;
    assert_eq!(
        spectrogram(&y, &good),
        Err(StftError::NotFinite {
            index: 42,
            value: f64::NEG_INFINITY
        })
    );
    assert_eq!(
        spectrogram(&x[..10], &good),
        Err(StftError::TooShort {
            samples: 10,
            segment_len: 20
        })
    );
    // paper L = N/15 < 2 for N < 30
    assert_eq!(
        spectrogram(&x[..29], &StftOptions::paper(29, 10.0)),
        Err(StftError::SegmentTooShort { segment_len: 1 })
    );
    assert_eq!(
        spectrogram(&x, &StftOptions::with_segments(100, 10.0, 0)),
        Err(StftError::SegmentTooShort { segment_len: 0 })
    );
    for ov in [1.0, -0.1, 1.5] {
        let mut o = good;
        o.overlap = ov;
        assert_eq!(
            spectrogram(&x, &o),
            Err(StftError::BadOverlap { overlap: ov })
        );
    }
    let mut o = good;
    o.overlap = f64::NAN;
    assert!(
        matches!(spectrogram(&x, &o), Err(StftError::BadOverlap { overlap }) if overlap.is_nan())
    );
    for fs in [0.0, -1.0, f64::INFINITY] {
        let o = StftOptions::with_segments(100, fs, 5);
        assert_eq!(
            spectrogram(&x, &o),
            Err(StftError::BadSampleRate { sample_rate: fs })
        );
    }
    let mut o = good;
    o.nfft = Some(19);
    assert_eq!(
        spectrogram(&x, &o),
        Err(StftError::BadNfft {
            nfft: 19,
            segment_len: 20
        })
    );
    // messages are one line and name the value
    let msg = StftError::BadOverlap { overlap: 1.5 }.to_string();
    assert!(msg.contains("1.5") && !msg.contains('\n'));

    // compare
    let a = spectrogram(&x, &good).unwrap();
    let b = spectrogram(&x, &StftOptions::with_segments(100, 10.0, 4)).unwrap();
    assert!(matches!(
        compare(&a, &b, 0.01),
        Err(StftError::ShapeMismatch { .. })
    ));
    let b = spectrogram(&x[..99], &good).unwrap();
    assert!(matches!(
        compare(&a, &b, 0.01),
        Err(StftError::ShapeMismatch {
            measured_time: 9,
            model_time: 8,
            ..
        })
    ));
    let mut ps = good;
    ps.scaling = Scaling::Psd;
    let b = spectrogram(&x, &ps).unwrap();
    assert_eq!(
        compare(&a, &b, 0.01),
        Err(StftError::ScalingMismatch {
            measured: Scaling::Amplitude,
            model: Scaling::Psd
        })
    );
    let b = spectrogram(&x, &StftOptions::with_segments(100, 20.0, 5)).unwrap();
    assert!(matches!(
        compare(&a, &b, 0.01),
        Err(StftError::GridMismatch {
            axis: "frequency",
            index: 1,
            ..
        })
    ));
    for fl in [-0.1, 1.5, f64::NAN] {
        assert!(matches!(
            compare(&a, &a, fl),
            Err(StftError::BadFloor { .. })
        ));
    }
    let zero = spectrogram(&vec![0.0; 100], &good).unwrap();
    assert_eq!(compare(&zero, &a, 0.01), Err(StftError::ZeroMeasured));
    let mut bad = a.clone();
    bad.magnitude[7] = -1.0;
    assert!(matches!(
        compare(&bad, &a, 0.01),
        Err(StftError::BadValue {
            which: "measured",
            t: 0,
            k: 7,
            ..
        })
    ));
    bad.magnitude.pop();
    assert!(matches!(
        compare(&a, &bad, 0.01),
        Err(StftError::ShapeMismatch { .. }) | Err(StftError::BadLayout { .. })
    ));
}

#[test]
fn huge_finite_values_keep_a_finite_amplitude() {
    // |X|² overflows for amplitudes ~1e200; the amplitude must not.
    let fs = 100.0;
    let x: Vec<f64> = (0..15_000)
        .map(|n| 1e200 * (2.0 * PI * 25.0 * n as f64 / fs).sin())
        .collect();
    let s = spectrogram(&x, &StftOptions::paper(x.len(), fs)).unwrap();
    assert_eq!(s.frequencies[250], 25.0);
    for t in 0..s.n_time {
        assert!(
            (s.at(t, 250) / 1e200 - 1.0).abs() < 1e-4,
            "{}",
            s.at(t, 250)
        );
    }
    assert!(s.magnitude.iter().all(|v| v.is_finite()));
}
