//! STFT spectrograms and their comparison (`nlsdof spectrogram`, paper
//! §4.5, Eq 33): the figure title, the JSON document and the text report.
//! The heat map and the waterfall are drawn by [`nlsdof_figure`].

use nlsdof::signal_processing::stft::{
    Detrend, Scaling, Spectrogram, SpectrogramDifference, StftLayout, StftOptions,
};
use nlsdof::signal_processing::Symmetry;
use serde_json::{json, Value};
use std::fmt::Write as _;

/// One spectrogram run, as its reports state it.
#[derive(Debug, Clone, Copy)]
pub struct SpectrogramRun<'a> {
    /// `file [column]` of the measured record.
    pub label: &'a str,
    /// The input file and its column.
    pub input: &'a str,
    pub column: &'a str,
    /// The comparison file and column, if any.
    pub compare: Option<(&'a str, &'a str)>,
    /// Sampling frequency (Hz), time of the first sample (s), samples.
    pub fs: f64,
    pub t0: f64,
    pub samples: usize,
    pub options: &'a StftOptions,
    pub layout: &'a StftLayout,
    /// The measured spectrogram (in the band).
    pub measured: &'a Spectrogram,
    /// Eq 33 and its robust variant, when compared.
    pub difference: Option<&'a SpectrogramDifference>,
    /// Floor of the robust variant, as a fraction of the measured maximum.
    pub floor: f64,
}

impl SpectrogramRun<'_> {
    fn symmetry(&self) -> &'static str {
        match self.options.symmetry {
            Symmetry::Periodic => "periodic",
            Symmetry::Symmetric => "symmetric",
        }
    }
}

/// A percentage for people: 3 decimals, scientific from 10^4 on, "inf".
fn fmt_percent(v: f64) -> String {
    if !v.is_finite() {
        "inf".into()
    } else if v.abs() >= 1e4 {
        format!("{v:.3e}")
    } else {
        format!("{v:.3}")
    }
}

fn json_num(v: f64) -> serde_json::Value {
    if v.is_finite() {
        json!(v)
    } else {
        json!(null)
    }
}

/// The title of the heat map and the waterfall: STFT layout and, when
/// compared, the Eq 33 maximum and its robust variant (%).
pub fn title(run: &SpectrogramRun) -> String {
    match run.difference {
        Some(d) => format!(
            "STFT, L = {}, {} % overlap, {} {} window; Eq 33 max = {} %, robust (>= {} of max) = {} %",
            run.layout.segment_len,
            (100.0 * run.layout.noverlap as f64 / run.layout.segment_len as f64).round(),
            run.symmetry(),
            run.options.window.name(),
            fmt_percent(d.max_relative_percent),
            run.floor,
            fmt_percent(d.robust_max_relative_percent)
        ),
        None => format!(
            "STFT, L = {}, {} % overlap, {} {} window",
            run.layout.segment_len,
            (100.0 * run.layout.noverlap as f64 / run.layout.segment_len as f64).round(),
            run.symmetry(),
            run.options.window.name()
        ),
    }
}

/// The peak of the measured spectrogram: value, time (s), frequency (Hz).
fn peak(sm: &Spectrogram) -> (f64, f64, f64) {
    let (pk_i, pk) =
        sm.magnitude.iter().enumerate().fold(
            (0, 0.0f64),
            |(bi, bv), (i, &v)| if v > bv { (i, v) } else { (bi, bv) },
        );
    (
        pk,
        sm.times[pk_i / sm.n_freq],
        sm.frequencies[pk_i % sm.n_freq],
    )
}

/// The JSON document of `nlsdof spectrogram --json`; `outputs` names the
/// files written, `timings` are the measured STFT, plotting and total
/// times (s).
pub fn json(run: &SpectrogramRun, outputs: Value, timings: (f64, f64, f64)) -> Value {
    let (pk, pk_t, pk_f) = peak(run.measured);
    json!({
        "input": run.input,
        "column": run.column,
        "samples": run.samples,
        "fs_hz": run.fs,
        "t0_s": run.t0,
        "stft": {
            "window": run.options.window.name(),
            "symmetry": run.symmetry(),
            "segment_len": run.layout.segment_len,
            "noverlap": run.layout.noverlap,
            "hop": run.layout.hop,
            "segments": run.layout.n_segments,
            "nfft": run.layout.nfft,
            "bins": run.layout.n_freq,
            "used_samples": run.layout.used_samples,
            "frequency_resolution_hz": run.fs / run.layout.nfft as f64,
            "time_step_s": run.layout.hop as f64 / run.fs,
            "detrend": match run.options.detrend { Detrend::None => "none", Detrend::Constant => "constant" },
            "scaling": run.options.scaling.name(),
        },
        "band_hz": [run.measured.frequencies[0], run.measured.frequencies[run.measured.n_freq - 1]],
        "band_bins": run.measured.n_freq,
        "peak": {"value": pk, "time_s": pk_t, "frequency_hz": pk_f},
        "compare": run.difference.map(|d| json!({
            "file": run.compare.map(|c| c.0),
            "column": run.compare.map(|c| c.1),
            "eq33_max_relative_percent": json_num(d.max_relative_percent),
            "eq33_infinite": d.max_relative_percent.is_infinite(),
            "eq33_at_time_s": d.at_time,
            "eq33_at_frequency_hz": d.at_frequency,
            "robust_max_relative_percent": json_num(d.robust_max_relative_percent),
            "floor_fraction": d.floor_fraction,
            "robust_at_time_s": d.robust_at_time,
            "robust_at_frequency_hz": d.robust_at_frequency,
            "bins_compared": d.bins_compared,
            "bins_total": d.bins_total,
            "global_relative_percent": json_num(d.global_relative_percent),
        })),
        "outputs": outputs,
        "stft_s": timings.0,
        "plot_s": timings.1,
        "total_s": timings.2,
    })
}

/// The text report of `nlsdof spectrogram`; `stft_s` is the measured STFT
/// time (s).
pub fn text(run: &SpectrogramRun, stft_s: f64) -> String {
    let (pk, pk_t, pk_f) = peak(run.measured);
    let unit = match run.options.scaling {
        Scaling::Amplitude => "(signal unit, 0-peak)",
        Scaling::Psd => "unit^2/Hz",
    };
    let mut s = String::new();
    writeln!(
                s,
            "{}: {} samples at {} Hz; STFT {} {} window, L = {}, overlap {} ({} segments, hop {:.4} s), {} bins every {:.6} Hz; {:.3} s",
            run.label,
            run.samples,
            run.fs,
            run.symmetry(),
            run.options.window.name(),
            run.layout.segment_len,
            run.layout.noverlap,
            run.layout.n_segments,
            run.layout.hop as f64 / run.fs,
            run.layout.n_freq,
            run.fs / run.layout.nfft as f64,
            stft_s
        ).ok();
    writeln!(
        s,
        "peak {} = {:.6e} {unit} at t = {:.3} s, f = {:.4} Hz (band {:.4}..{:.4} Hz)",
        run.options.scaling.name(),
        pk,
        pk_t,
        pk_f,
        run.measured.frequencies[0],
        run.measured.frequencies[run.measured.n_freq - 1]
    )
    .ok();
    if let Some(d) = run.difference {
        writeln!(
            s,
            "Eq 33 max |s_exp - s_num|/s_exp = {} % at t = {:.3} s, f = {:.4} Hz (all {} bins)",
            fmt_percent(d.max_relative_percent),
            d.at_time,
            d.at_frequency,
            d.bins_total
        )
        .ok();
        writeln!(
                s,
                "robust (s_exp >= {} x max): {} % at t = {:.3} s, f = {:.4} Hz ({} of {} bins); global ||s_exp - s_num||/||s_exp|| = {:.4} %",
                d.floor_fraction,
                fmt_percent(d.robust_max_relative_percent),
                d.robust_at_time,
                d.robust_at_frequency,
                d.bins_compared,
                d.bins_total,
                d.global_relative_percent
            ).ok();
    }
    s
}
