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
//!
//! **Coulomb friction** (`κ > 0`, `η = −1`) converges only like `1/n`
//! ([`super::extrapolation`]; `n` the harmonics carrying the response, the
//! odd ones under half-wave symmetry): the change between two rows then
//! understates the error of the last (by `n₁/(n₂ − n₁)`, e.g. 2 from H = 3
//! to 5). For such models every pair of consecutive rows is extrapolated
//! in `n` (Richardson: peak frequency, amplitude, `max|x|` and folds), the
//! study stops when two successive extrapolations agree to `tol`, and the
//! last extrapolation is the reference ([`TruncationStudy::extrapolated`]).

use super::continuation::{continue_in_omega, ContinuationOptions};
use super::extrapolation::{effective_harmonics, richardson};
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
    /// changed, NaN for the first row). With Coulomb friction (module
    /// docs): the change of the extrapolation ending at this row from the
    /// one ending at the previous row (NaN for the first two rows).
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
    /// With Coulomb friction (module docs): the Richardson extrapolation in
    /// the number of harmonics of the reference row and the row before it
    /// (its `harmonics` is the reference row's H, `samples` and `points`
    /// are the reference row's); the errors of the rows are measured
    /// against it. `None` for every other model, or with fewer than two
    /// rows.
    pub extrapolated: Option<TruncationRow>,
}

/// Richardson extrapolation in the effective harmonic counts `(n_a, n_b)`
/// of two rows (every quantity `Q(n) = Q∞ + c/n`); `None` if the rows do
/// not have the same peaks and folds.
fn extrapolate(
    a: &TruncationRow,
    na: usize,
    b: &TruncationRow,
    nb: usize,
) -> Option<TruncationRow> {
    if a.folds.len() != b.folds.len() || a.peak.is_some() != b.peak.is_some() || na == nb {
        return None;
    }
    let r = |x: f64, y: f64| richardson(na, x, nb, y).ok();
    let peak = match (a.peak, b.peak) {
        (Some(p), Some(q)) => Some((r(p.0, q.0)?, r(p.1, q.1)?, r(p.2, q.2)?)),
        _ => None,
    };
    let folds = a
        .folds
        .iter()
        .zip(&b.folds)
        .map(|(f, g)| Some((r(f.0, g.0)?, r(f.1, g.1)?)))
        .collect::<Option<Vec<_>>>()?;
    Some(TruncationRow {
        harmonics: b.harmonics,
        peak,
        folds,
        samples: b.samples,
        points: b.points,
        change: f64::NAN,
        warning: None,
    })
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
    let coulomb = model.kappa > 0.0 && model.eta == -1.0;
    let mut rows: Vec<TruncationRow> = Vec::new();
    // effective harmonic counts of the rows, and the extrapolations (Coulomb)
    let mut counts: Vec<usize> = Vec::new();
    let mut extrapolations: Vec<Option<TruncationRow>> = Vec::new();
    for &h in harmonics {
        let br = continue_in_omega(model, gamma, h, omega_min, omega_max, settings, opts)?;
        let peak_point = br
            .peaks
            .iter()
            .max_by(|a, b| a.amplitude(1).total_cmp(&b.amplitude(1)));
        counts.push(peak_point.map_or(h, |p| effective_harmonics(&p.coefficients, h)));
        let peak = peak_point.map(|p| {
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
            let k = rows.len();
            if coulomb {
                let e = extrapolate(prev, counts[k - 1], &row, counts[k]);
                row.change = match (&e, extrapolations.last()) {
                    (Some(e), Some(Some(p))) => row_difference(e, p),
                    (None, _) => f64::INFINITY,
                    _ => f64::NAN,
                };
                extrapolations.push(e);
            } else {
                row.change = row_difference(&row, prev);
            }
        }
        let done = row.change <= tol && row.warning.is_none();
        rows.push(row);
        if done {
            break;
        }
    }
    let reference = rows.len() - 1;
    let converged = rows[reference].change <= tol && rows[reference].warning.is_none();
    Ok(TruncationStudy {
        rows,
        reference,
        converged,
        extrapolated: extrapolations.pop().flatten(),
    })
}
