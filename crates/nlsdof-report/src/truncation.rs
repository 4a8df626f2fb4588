//! How wrong the first-order harmonic balance is (`nlsdof hb-error`,
//! [`nlsdof::multi_harmonic::truncation`]): per level and number of
//! harmonics H, the resonance peak and the folds, with their errors
//! relative to the converged H, as JSON and text.

use nlsdof::multi_harmonic::truncation::{TruncationRow, TruncationStudy};
use nlsdof::Model;
use serde_json::{json, Value};
use std::f64::consts::PI;
use std::fmt::Write as _;

/// What the study was asked for, as its reports state it.
#[derive(Debug, Clone, Copy)]
pub struct StudyRequest<'a> {
    /// The model's name (its file).
    pub model_name: &'a str,
    /// Band, Hz.
    pub f_min: f64,
    pub f_max: f64,
    /// Convergence tolerance (relative).
    pub tol: f64,
}

fn hz(w: f64) -> f64 {
    w / (2.0 * PI)
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The row the errors are measured against: the extrapolation in H
/// (Coulomb friction) when the study made one, else the reference H.
fn reference_row(st: &TruncationStudy) -> &TruncationRow {
    st.extrapolated.as_ref().unwrap_or(&st.rows[st.reference])
}

/// The lower H of the extrapolation (the row before the reference).
fn extrapolated_from(st: &TruncationStudy) -> usize {
    st.rows[st.reference.saturating_sub(1)].harmonics
}

fn errors(st: &TruncationStudy, i: usize) -> (Option<f64>, Option<f64>, Vec<Option<f64>>) {
    let r = &st.rows[i];
    let reference = reference_row(st);
    let (pa, pf) = match (r.peak, reference.peak) {
        (Some(p), Some(q)) => (Some(rel(p.1, q.1)), Some(rel(p.0, q.0))),
        _ => (None, None),
    };
    let folds = if r.folds.len() == reference.folds.len() {
        r.folds
            .iter()
            .zip(&reference.folds)
            .map(|(a, b)| Some(rel(a.0, b.0)))
            .collect()
    } else {
        r.folds.iter().map(|_| None).collect()
    };
    (pa, pf, folds)
}

/// The JSON document of `nlsdof hb-error --json`; `studies` pairs each
/// level γ (m/s², zero-to-peak) with its study.
pub fn study_json(req: &StudyRequest, model: &Model, studies: &[(f64, TruncationStudy)]) -> Value {
    let levels: Vec<_> = studies
        .iter()
        .map(|(g, st)| {
            let rows: Vec<_> = st
                .rows
                .iter()
                .enumerate()
                .map(|(i, r)| {
                    let (pa, pf, fe) = errors(st, i);
                    json!({
                        "harmonics": r.harmonics,
                        "peak": r.peak.map(|p| json!({"f_hz": hz(p.0), "amplitude": p.1, "max_abs_x": p.2})),
                        "folds_hz": r.folds.iter().map(|f| hz(f.0)).collect::<Vec<_>>(),
                        "fold_amplitudes": r.folds.iter().map(|f| f.1).collect::<Vec<_>>(),
                        "peak_amplitude_error": pa,
                        "peak_frequency_error": pf,
                        "fold_frequency_errors": fe,
                        "change": if r.change.is_finite() { Some(r.change) } else { None },
                        "samples_per_period": r.samples,
                        "points": r.points,
                        "warning": r.warning.as_ref().map(|w| w.to_string()),
                    })
                })
                .collect();
            json!({
                "gamma": g,
                "converged": st.converged,
                "reference_harmonics": st.rows[st.reference].harmonics,
                // Coulomb friction: Richardson extrapolation in H of the
                // last two rows, the reference of the errors
                "extrapolated": st.extrapolated.as_ref().map(|r| json!({
                    "from_harmonics": [extrapolated_from(st), r.harmonics],
                    "peak": r.peak.map(|p| json!({"f_hz": hz(p.0), "amplitude": p.1, "max_abs_x": p.2})),
                    "folds_hz": r.folds.iter().map(|f| hz(f.0)).collect::<Vec<_>>(),
                })),
                "rows": rows,
            })
        })
        .collect();
    json!({
        "model": req.model_name,
        "f_n_hz": hz(model.omega_n()),
        "f_min_hz": req.f_min,
        "f_max_hz": req.f_max,
        "tol": req.tol,
        "units": {"gamma": "m/s^2 zero-to-peak", "amplitude": "m zero-to-peak (first harmonic)", "errors": "relative, against the reference H (Coulomb friction: against the extrapolation in H)"},
        "levels": levels,
    })
}

/// The text report of `nlsdof hb-error`: one table per level.
pub fn study_text(req: &StudyRequest, model: &Model, studies: &[(f64, TruncationStudy)]) -> String {
    let (f_min, f_max) = (req.f_min, req.f_max);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "model {}: {}",
        req.model_name,
        crate::steady_state::model_summary(model)
    );
    let _ = writeln!(
        s,
        "band {f_min} .. {f_max} Hz; errors relative to the converged H (tol {:e}); amplitudes zero-to-peak, first harmonic",
        req.tol
    );
    for (g, st) in studies {
        let _ = writeln!(s);
        let reference = &st.rows[st.reference];
        let _ = writeln!(
            s,
            "gamma = {g} m/s^2: {} at H = {}",
            if st.converged {
                "converged"
            } else {
                "NOT converged, errors against"
            },
            reference.harmonics
        );
        if let Some(x) = &st.extrapolated {
            let h0 = extrapolated_from(st);
            let peak = x.peak.map_or("no peak".into(), |p| {
                format!("peak a1 {:.7e} m at {:.8} Hz", p.1, hz(p.0))
            });
            let _ = writeln!(
                s,
                "  Coulomb friction: HB converges only like 1/H; errors are against the Richardson \
                 extrapolation of H = {h0} and {}: {peak}{}",
                x.harmonics,
                if x.folds.is_empty() {
                    String::new()
                } else {
                    format!(
                        ", folds {}",
                        x.folds
                            .iter()
                            .map(|f| format!("{:.8} Hz", hz(f.0)))
                            .collect::<Vec<_>>()
                            .join(", ")
                    )
                }
            );
        }
        let _ = writeln!(
            s,
            "   H   peak a1 [m]    peak f [Hz]   max|x| [m]     err a1     err f_peak  folds [Hz] (err)                     N"
        );
        for (i, r) in st.rows.iter().enumerate() {
            let (pa, pf, fe) = errors(st, i);
            let peak = match r.peak {
                Some(p) => format!("{:.6e}  {:<12.7}  {:.6e}", p.1, hz(p.0), p.2),
                None => format!("{:<40}", "no peak in the band"),
            };
            let e = |v: Option<f64>| v.map(|x| format!("{x:.2e}")).unwrap_or_else(|| "-".into());
            let folds: Vec<String> = r
                .folds
                .iter()
                .zip(&fe)
                .map(|(f, err)| format!("{:.7} ({})", hz(f.0), e(*err)))
                .collect();
            let _ = writeln!(
                s,
                "{:4}   {peak}   {:>9}  {:>9}   {:<38} {}",
                r.harmonics,
                e(pa),
                e(pf),
                if folds.is_empty() {
                    "none".into()
                } else {
                    folds.join(", ")
                },
                r.samples
            );
        }
    }
    s
}
