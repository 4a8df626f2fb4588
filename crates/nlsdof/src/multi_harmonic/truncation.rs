//! How wrong is first order? The truncation error of the harmonic balance
//! in the resonance peak and the fold frequencies, against the number of
//! harmonics H, until it converges.
//!
//! For each H of an increasing list the branch over `[Ω_min, Ω_max]` is
//! continued ([`super::continuation`]); from it are taken the located
//! first-harmonic peak (amplitude, frequency, `max|x|` there) and the
//! located folds. The study stops at the first H whose change from the
//! previous H is at most `tol` (relative) in the peak amplitude, the peak
//! frequency and every fold frequency, with the same number of folds; that
//! H is the reference and every row's error is measured against it. If
//! the list ends first, the study is reported as not converged (the last
//! change is given).

use super::continuation::{continue_in_omega, ContinuationOptions};
use super::system::HarmonicSettings;
use super::{max_abs_displacement, MhbError};
use crate::model::AsNormalised;

/// One H.
#[derive(Debug, Clone, PartialEq)]
pub struct TruncationRow {
    pub harmonics: usize,
    /// Located peak of the first-harmonic amplitude (largest if several):
    /// (Ω rad/s, amplitude m, max|x| m). `None` if the branch has no maximum.
    pub peak: Option<(f64, f64, f64)>,
    /// Fold frequencies (rad/s) and first-harmonic amplitudes (m), increasing Ω.
    pub folds: Vec<(f64, f64)>,
    /// Samples per period used.
    pub samples: usize,
    /// Points of the branch.
    pub points: usize,
    /// Largest relative change from the previous row (∞ if the fold count
    /// changed, NaN for the first row).
    pub change: f64,
    /// Set if the continuation stopped early.
    pub warning: Option<MhbError>,
}

/// Result of [`truncation_study`].
#[derive(Debug, Clone, PartialEq)]
pub struct TruncationStudy {
    pub rows: Vec<TruncationRow>,
    /// Index of the reference row (the converged H, or the last row).
    pub reference: usize,
    pub converged: bool,
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(f64::MIN_POSITIVE)
}

/// Largest relative difference of peak and folds between two rows (∞ if
/// not comparable).
pub fn row_difference(a: &TruncationRow, b: &TruncationRow) -> f64 {
    if a.folds.len() != b.folds.len() || a.peak.is_some() != b.peak.is_some() {
        return f64::INFINITY;
    }
    let mut d: f64 = 0.0;
    if let (Some(p), Some(q)) = (a.peak, b.peak) {
        d = d.max(rel(p.0, q.0)).max(rel(p.1, q.1));
    }
    for (f, g) in a.folds.iter().zip(&b.folds) {
        d = d.max(rel(f.0, g.0));
    }
    d
}

/// The harmonic counts `nlsdof hb-error` (and the Python `hb_error`) try,
/// in order: odd first, since symmetric power laws excite odd harmonics
/// (the even ones are part of every balance and stay zero there).
pub const HARMONIC_LADDER: [usize; 12] = [1, 3, 5, 7, 9, 11, 15, 21, 31, 41, 51, 63];

/// The study for `harmonics` (increasing, each ≥ 1), see the module docs.
/// A model without any damping is refused ([`MhbError::Undamped`]).
pub fn truncation_study(
    model: &(impl AsNormalised + ?Sized),
    gamma: f64,
    omega_min: f64,
    omega_max: f64,
    harmonics: &[usize],
    tol: f64,
    settings: HarmonicSettings,
    opts: &ContinuationOptions,
) -> Result<TruncationStudy, MhbError> {
    let model = &model.as_normalised()?;
    if model.delta == 0.0 && model.kappa == 0.0 {
        return Err(MhbError::Undamped);
    }
    if !(tol.is_finite() && tol > 0.0) {
        return Err(MhbError::InvalidValue {
            name: "tol",
            value: tol,
        });
    }
    if harmonics.is_empty() {
        return Err(MhbError::InvalidValue {
            name: "number of harmonic counts",
            value: 0.0,
        });
    }
    let mut rows: Vec<TruncationRow> = Vec::new();
    for &h in harmonics {
        let br = continue_in_omega(model, gamma, h, omega_min, omega_max, settings, opts)?;
        let peak = br
            .peaks
            .iter()
            .max_by(|a, b| a.amplitude(1).total_cmp(&b.amplitude(1)))
            .map(|p| {
                (
                    p.omega,
                    p.amplitude(1),
                    max_abs_displacement(&p.coefficients),
                )
            });
        let mut folds: Vec<(f64, f64)> = br
            .limit_points
            .iter()
            .map(|l| (l.point.omega, l.point.amplitude(1)))
            .collect();
        folds.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut row = TruncationRow {
            harmonics: h,
            peak,
            folds,
            samples: br.samples,
            points: br.points.len(),
            change: f64::NAN,
            warning: br.warning,
        };
        if let Some(prev) = rows.last() {
            row.change = row_difference(&row, prev);
        }
        let done = row.change <= tol && row.warning.is_none();
        rows.push(row);
        if done {
            let reference = rows.len() - 1;
            return Ok(TruncationStudy {
                rows,
                reference,
                converged: true,
            });
        }
    }
    let reference = rows.len() - 1;
    Ok(TruncationStudy {
        rows,
        reference,
        converged: false,
    })
}
