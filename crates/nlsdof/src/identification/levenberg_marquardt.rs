//! Bounded Levenberg–Marquardt for small dense least-squares problems.
//!
//! Minimises `‖r(u)‖²` subject to `lo ≤ u ≤ hi`. Each iteration solves the
//! damped normal equations `(JᵀJ + λ diag(JᵀJ)) δ = −Jᵀr` on the variables
//! not held by an active bound (a variable at a bound whose gradient points
//! out of the box is frozen for the step), projects `u + δ` onto the box and
//! accepts it if the cost decreases. λ follows Nielsen's update rule
//! (gain ratio of the actual to the linear-model reduction).

use std::fmt;

/// A least-squares problem: residuals and their Jacobian (row-major, one row
/// per residual). `None` means "not evaluable here" (the step is rejected).
pub trait LeastSquares: Sync {
    fn n_params(&self) -> usize;
    fn residuals(&self, u: &[f64]) -> Option<Vec<f64>>;
    fn residuals_and_jacobian(&self, u: &[f64]) -> Option<(Vec<f64>, Vec<f64>)>;
    /// `true` when [`Self::residuals_and_jacobian`] costs little more than
    /// [`Self::residuals`] (analytic derivatives of an expensive model, as
    /// the branch-following sweeps of Eq 31): [`minimise`] then evaluates
    /// the Jacobian with every trial step and keeps it when the step is
    /// accepted, instead of evaluating the accepted point a second time.
    /// The iterates, counts and stopping rules are the same either way.
    fn jacobian_with_trials(&self) -> bool {
        false
    }
}

/// Stopping rules.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LmOptions {
    pub max_iterations: usize,
    /// Stop after this many objective evaluations (a discontinuous
    /// objective — a jump moving across a step — can make LM reject many steps).
    pub max_evaluations: usize,
    /// Stop when every accepted step satisfies `|δ_k| ≤ xtol (1 + |u_k|)`.
    pub xtol: f64,
    /// Stop when an accepted step reduces the cost by less than `ftol · cost`.
    pub ftol: f64,
    /// Stop when the cosine between the residual and every free Jacobian
    /// column is below `gtol`.
    pub gtol: f64,
    /// Stop when the cost is at most this (an exact fit).
    pub cost_floor: f64,
    /// Stop when the Gauss–Newton step on the free variables would lower
    /// the cost by at most `decrement_tol · s²` (`s² = cost/(m − n)`, m
    /// residuals, n parameters): the optimum is then within
    /// `√decrement_tol` standard errors (in the metric of `JᵀJ`), far
    /// inside the statistical resolution of the estimate; or when the last
    /// [`PROGRESS_WINDOW`] accepted steps lowered it by less than
    /// `100 · decrement_tol · s²` in all (a crawl along a ridge of the cost
    /// whose floor is flat to the resolution of the data). 0 (default) = off.
    pub decrement_tol: f64,
    /// Polled before every evaluation: once set, [`minimise`] stops at
    /// once (termination [`Termination::MaxIterations`]; the callers turn
    /// that into their *interrupted* error, [`crate::cancel`]).
    pub cancel: crate::cancel::Cancel,
}

impl Default for LmOptions {
    fn default() -> Self {
        Self {
            max_iterations: 100,
            max_evaluations: 300,
            xtol: 1e-12,
            ftol: 1e-14,
            gtol: 1e-12,
            cost_floor: 0.0,
            decrement_tol: 0.0,
            cancel: crate::cancel::Cancel::NEVER,
        }
    }
}

/// Accepted steps over which [`LmOptions::decrement_tol`]'s progress test
/// looks back.
pub const PROGRESS_WINDOW: usize = 5;

/// Why the iteration stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Termination {
    /// The cost reached `cost_floor` (exact fit).
    ZeroResidual,
    /// Relative step below `xtol`.
    SmallStep,
    /// Relative cost reduction below `ftol`.
    SmallCostReduction,
    /// Projected gradient (cosine) below `gtol`.
    SmallGradient,
    /// `max_iterations` or `max_evaluations` reached.
    MaxIterations,
    /// No decrease found even with a very large damping (λ > 1e20).
    Stalled,
    /// The Gauss–Newton decrement, or the progress of the last steps, is
    /// below the statistical resolution ([`LmOptions::decrement_tol`]).
    SmallDecrement,
}

impl Termination {
    pub fn name(self) -> &'static str {
        match self {
            Termination::ZeroResidual => "zero-residual",
            Termination::SmallStep => "small-step",
            Termination::SmallCostReduction => "small-cost-reduction",
            Termination::SmallGradient => "small-gradient",
            Termination::MaxIterations => "max-iterations",
            Termination::Stalled => "stalled",
            Termination::SmallDecrement => "small-decrement",
        }
    }

    /// Whether this is a convergence criterion (not a give-up).
    pub fn converged(self) -> bool {
        !matches!(self, Termination::MaxIterations | Termination::Stalled)
    }
}

impl fmt::Display for Termination {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Result of one local minimisation.
#[derive(Debug, Clone, PartialEq)]
pub struct LmResult {
    pub u: Vec<f64>,
    pub cost: f64,
    pub iterations: usize,
    pub evaluations: usize,
    pub termination: Termination,
}

/// The start point cannot be evaluated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("the objective cannot be evaluated at the start point {start:?}")]
pub struct StartNotEvaluable {
    pub start: Vec<f64>,
}

fn sum_sq(r: &[f64]) -> f64 {
    r.iter().map(|x| x * x).sum()
}

/// Solves the symmetric positive definite system `a x = b` (n × n,
/// row-major) by Cholesky; `None` if not positive definite.
pub(crate) fn cholesky_solve(a: &[f64], b: &[f64], n: usize) -> Option<Vec<f64>> {
    let mut l = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= l[i * n + k] * l[j * n + k];
            }
            if i == j {
                if !(s > 0.0) || !s.is_finite() {
                    return None;
                }
                l[i * n + i] = s.sqrt();
            } else {
                l[i * n + j] = s / l[j * n + j];
            }
        }
    }
    let mut y = b.to_vec();
    for i in 0..n {
        for k in 0..i {
            y[i] -= l[i * n + k] * y[k];
        }
        y[i] /= l[i * n + i];
    }
    for i in (0..n).rev() {
        for k in i + 1..n {
            y[i] -= l[k * n + i] * y[k];
        }
        y[i] /= l[i * n + i];
    }
    Some(y)
}

/// `(JᵀJ, Jᵀr)` for row-major `J` (m × n).
pub fn normal_equations(j: &[f64], r: &[f64], n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut a = vec![0.0; n * n];
    let mut g = vec![0.0; n];
    for (row, &ri) in j.chunks_exact(n).zip(r) {
        for p in 0..n {
            let jp = row[p];
            if jp == 0.0 {
                continue;
            }
            g[p] += jp * ri;
            for q in 0..=p {
                a[p * n + q] += jp * row[q];
            }
        }
    }
    for p in 0..n {
        for q in 0..p {
            a[q * n + p] = a[p * n + q];
        }
    }
    (a, g)
}

/// Bounded Levenberg–Marquardt from `u0` (projected onto the box).
pub fn minimise<P: LeastSquares + ?Sized>(
    problem: &P,
    u0: &[f64],
    lo: &[f64],
    hi: &[f64],
    opts: &LmOptions,
) -> Result<LmResult, StartNotEvaluable> {
    minimise_resumable(problem, u0, lo, hi, opts, LmState::default()).map(|(r, _)| r)
}

/// What [`minimise`] carries from one iteration to the next besides the
/// point: the damping λ, its growth factor ν and the costs after the last
/// accepted steps (the progress test of [`LmOptions::decrement_tol`]).
/// [`minimise_resumable`] returns it, so that a run stopped by
/// `max_iterations` can be continued from its point as if it had not
/// stopped.
#[derive(Debug, Clone, PartialEq)]
pub struct LmState {
    pub lambda: f64,
    pub nu: f64,
    history: std::collections::VecDeque<f64>,
}

impl Default for LmState {
    /// The state [`minimise`] starts from.
    fn default() -> Self {
        Self {
            lambda: 1e-3,
            nu: 2.0,
            history: std::collections::VecDeque::new(),
        }
    }
}

/// [`minimise`] from a given [`LmState`], returning the state at the stop.
/// Continuing a run that stopped at `max_iterations` (from its `u`, with
/// its state and the rest of the budget) gives the iterates the run would
/// have taken without the stop (one more evaluation: the Jacobian at the
/// restart point). [`minimise`] is this from [`LmState::default`].
pub fn minimise_resumable<P: LeastSquares + ?Sized>(
    problem: &P,
    u0: &[f64],
    lo: &[f64],
    hi: &[f64],
    opts: &LmOptions,
    state: LmState,
) -> Result<(LmResult, LmState), StartNotEvaluable> {
    let n = problem.n_params();
    let clamp = |v: f64, k: usize| v.max(lo[k]).min(hi[k]);
    let mut u: Vec<f64> = (0..n).map(|k| clamp(u0[k], k)).collect();
    if opts.cancel.is_cancelled() {
        // cancelled before the first evaluation: no start evaluated (the
        // callers report the interruption, `LmOptions::cancel`)
        return Err(StartNotEvaluable { start: u });
    }
    let (mut r, mut j) = problem
        .residuals_and_jacobian(&u)
        .ok_or_else(|| StartNotEvaluable { start: u.clone() })?;
    let mut evaluations = 1;
    let mut cost = sum_sq(&r);
    let LmState {
        mut lambda,
        mut nu,
        // costs after the last accepted steps (the progress test)
        mut history,
    } = state;
    let mut iterations = 0;
    macro_rules! done {
        ($u:expr, $cost:expr, $iterations:expr, $evaluations:expr, $termination:expr $(,)?) => {
            Ok((
                LmResult {
                    u: $u,
                    cost: $cost,
                    iterations: $iterations,
                    evaluations: $evaluations,
                    termination: $termination,
                },
                LmState {
                    lambda,
                    nu,
                    history,
                },
            ))
        };
    }
    loop {
        if cost <= opts.cost_floor {
            return done!(u, cost, iterations, evaluations, Termination::ZeroResidual);
        }
        if iterations >= opts.max_iterations || opts.cancel.is_cancelled() {
            return done!(u, cost, iterations, evaluations, Termination::MaxIterations);
        }
        iterations += 1;
        let (a, g) = normal_equations(&j, &r, n);
        let active: Vec<bool> = (0..n)
            .map(|k| (u[k] <= lo[k] && g[k] > 0.0) || (u[k] >= hi[k] && g[k] < 0.0))
            .collect();
        let inactive: Vec<usize> = (0..n).filter(|&k| !active[k]).collect();
        let gnorm = inactive
            .iter()
            .map(|&k| {
                let d = (a[k * n + k] * cost).sqrt();
                if d > 0.0 {
                    g[k].abs() / d
                } else {
                    0.0
                }
            })
            .fold(0.0, f64::max);
        if inactive.is_empty() || gnorm <= opts.gtol {
            return done!(u, cost, iterations, evaluations, Termination::SmallGradient);
        }
        let m = inactive.len();
        if opts.decrement_tol > 0.0 && r.len() > n {
            // Gauss–Newton decrement gᵀ A⁻¹ g on the free variables
            let mut ar = vec![0.0; m * m];
            let mut br = vec![0.0; m];
            for (p, &kp) in inactive.iter().enumerate() {
                for (q, &kq) in inactive.iter().enumerate() {
                    ar[p * m + q] = a[kp * n + kq];
                }
                br[p] = -g[kp];
            }
            if let Some(x) = cholesky_solve(&ar, &br, m) {
                let dec: f64 = -x.iter().zip(&br).map(|(x, b)| x * -b).sum::<f64>();
                let s2 = cost / (r.len() - n) as f64;
                if dec.is_finite() && dec.abs() <= opts.decrement_tol * s2 {
                    return done!(
                        u,
                        cost,
                        iterations,
                        evaluations,
                        Termination::SmallDecrement,
                    );
                }
            }
        }
        loop {
            let mut ar = vec![0.0; m * m];
            let mut br = vec![0.0; m];
            let mut dmax = 0.0f64;
            for &kp in &inactive {
                dmax = dmax.max(a[kp * n + kp]);
            }
            for (p, &kp) in inactive.iter().enumerate() {
                for (q, &kq) in inactive.iter().enumerate() {
                    ar[p * m + q] = a[kp * n + kq];
                }
                let diag = a[kp * n + kp].max(1e-12 * dmax).max(f64::MIN_POSITIVE);
                ar[p * m + p] += lambda * diag;
                br[p] = -g[kp];
            }
            let Some(step_r) = cholesky_solve(&ar, &br, m) else {
                lambda *= nu;
                nu *= 2.0;
                if lambda > 1e20 {
                    return done!(u, cost, iterations, evaluations, Termination::Stalled);
                }
                continue;
            };
            let mut un = u.clone();
            for (p, &k) in inactive.iter().enumerate() {
                un[k] = clamp(u[k] + step_r[p], k);
            }
            let step: Vec<f64> = (0..n).map(|k| un[k] - u[k]).collect();
            let small = (0..n).all(|k| step[k].abs() <= opts.xtol * (1.0 + u[k].abs()));
            if small {
                return done!(u, cost, iterations, evaluations, Termination::SmallStep);
            }
            // linear-model prediction
            let mut lin = 0.0;
            for (row, &ri) in j.chunks_exact(n).zip(&r) {
                let v = ri + row.iter().zip(&step).map(|(a, b)| a * b).sum::<f64>();
                lin += v * v;
            }
            let pred = cost - lin;
            if evaluations >= opts.max_evaluations || opts.cancel.is_cancelled() {
                return done!(u, cost, iterations, evaluations, Termination::MaxIterations);
            }
            evaluations += 1;
            // with the Jacobian when the problem asks for it (kept below if
            // the step is accepted); residuals alone if that fails, so that
            // the iterates do not depend on the choice
            let joint = problem
                .jacobian_with_trials()
                .then(|| problem.residuals_and_jacobian(&un))
                .flatten();
            let cost_new = match &joint {
                Some((rn, _)) => Some(sum_sq(rn)),
                None => problem.residuals(&un).map(|t| sum_sq(&t)),
            }
            .unwrap_or(f64::INFINITY);
            if cost_new < cost {
                let rho = if pred > 0.0 {
                    (cost - cost_new) / pred
                } else {
                    0.5
                };
                lambda *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
                lambda = lambda.max(1e-15);
                nu = 2.0;
                let reduction = cost - cost_new;
                let Some((rn, jn)) = joint.or_else(|| problem.residuals_and_jacobian(&un)) else {
                    lambda *= 4.0;
                    continue;
                };
                // (counted as an evaluation either way: same stopping rules)
                evaluations += 1;
                u = un;
                r = rn;
                j = jn;
                let old = cost;
                cost = cost_new;
                if cost <= opts.cost_floor {
                    return done!(u, cost, iterations, evaluations, Termination::ZeroResidual);
                }
                if opts.decrement_tol > 0.0 && r.len() > n {
                    history.push_back(old);
                    if history.len() > PROGRESS_WINDOW {
                        history.pop_front();
                    }
                    let s2 = cost / (r.len() - n) as f64;
                    if history.len() == PROGRESS_WINDOW
                        && history[0] - cost <= 100.0 * opts.decrement_tol * s2
                    {
                        return done!(
                            u,
                            cost,
                            iterations,
                            evaluations,
                            Termination::SmallDecrement,
                        );
                    }
                }
                if reduction <= opts.ftol * old {
                    return done!(
                        u,
                        cost,
                        iterations,
                        evaluations,
                        Termination::SmallCostReduction,
                    );
                }
                break;
            }
            lambda *= nu;
            nu *= 2.0;
            if lambda > 1e20 {
                return done!(u, cost, iterations, evaluations, Termination::Stalled);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock as least squares: r = (10(u1 − u0²), 1 − u0).
    struct Rosen;
    impl LeastSquares for Rosen {
        fn n_params(&self) -> usize {
            2
        }
        fn residuals(&self, u: &[f64]) -> Option<Vec<f64>> {
            Some(vec![10.0 * (u[1] - u[0] * u[0]), 1.0 - u[0]])
        }
        fn residuals_and_jacobian(&self, u: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
            Some((self.residuals(u)?, vec![-20.0 * u[0], 10.0, -1.0, 0.0]))
        }
    }

    #[test]
    fn rosenbrock_unbounded_and_bounded() {
        let inf = f64::INFINITY;
        let r = minimise(
            &Rosen,
            &[-1.2, 1.0],
            &[-inf, -inf],
            &[inf, inf],
            &LmOptions::default(),
        )
        .unwrap();
        assert!(
            (r.u[0] - 1.0).abs() < 1e-10 && (r.u[1] - 1.0).abs() < 1e-10,
            "{r:?}"
        );
        assert!(r.termination.converged());
        // bound u0 <= 0.5: optimum on the bound, u1 = 0.25
        let r = minimise(
            &Rosen,
            &[-1.2, 1.0],
            &[-inf, -inf],
            &[0.5, inf],
            &LmOptions::default(),
        )
        .unwrap();
        assert!(
            (r.u[0] - 0.5).abs() < 1e-12 && (r.u[1] - 0.25).abs() < 1e-8,
            "{r:?}"
        );
    }

    /// Rosenbrock asking for the Jacobian with every trial step, and
    /// counting its evaluations; its Jacobian fails in a band of `u0` that
    /// an accepted point of the unbounded run lies in (a trial there falls
    /// back to the residuals alone, and the step is then retried with a
    /// larger λ, as without the joint evaluation).
    struct RosenJoint {
        joint: bool,
        residual_calls: std::sync::atomic::AtomicUsize,
        jacobian_calls: std::sync::atomic::AtomicUsize,
    }
    impl LeastSquares for RosenJoint {
        fn n_params(&self) -> usize {
            2
        }
        fn residuals(&self, u: &[f64]) -> Option<Vec<f64>> {
            self.residual_calls
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            Rosen.residuals(u)
        }
        fn residuals_and_jacobian(&self, u: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
            self.jacobian_calls
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            if (0.32..0.33).contains(&u[0]) {
                return None;
            }
            Rosen.residuals_and_jacobian(u)
        }
        fn jacobian_with_trials(&self) -> bool {
            self.joint
        }
    }

    /// Evaluating the Jacobian with the trial steps changes no iterate,
    /// count or stopping rule; it only saves the second evaluation of every
    /// accepted point.
    #[test]
    fn jacobian_with_trials_gives_the_same_iterates() {
        use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
        let inf = f64::INFINITY;
        let run = |joint: bool, hi: f64| {
            let p = RosenJoint {
                joint,
                residual_calls: AtomicUsize::new(0),
                jacobian_calls: AtomicUsize::new(0),
            };
            let r = minimise(
                &p,
                &[-1.2, 1.0],
                &[-inf, -inf],
                &[hi, inf],
                &LmOptions::default(),
            )
            .unwrap();
            (
                r,
                p.residual_calls.load(Relaxed),
                p.jacobian_calls.load(Relaxed),
            )
        };
        for hi in [inf, 0.5] {
            let (a, ra, ja) = run(false, hi);
            let (b, rb, jb) = run(true, hi);
            assert_eq!(a, b);
            eprintln!("bound {hi}: separate {ra} residuals + {ja} Jacobians, joint {rb} + {jb}");
            // joint: a residual call only where the Jacobian failed
            assert!(rb < ra && ra + ja > rb + jb, "{ra} {ja} {rb} {jb}");
            if hi == inf {
                assert!(rb > 0, "the failing band was not visited");
            }
        }
    }

    /// A run stopped at `max_iterations` and continued with its state takes
    /// the iterates of the run that did not stop.
    #[test]
    fn resumed_run_takes_the_same_iterates() {
        let inf = f64::INFINITY;
        for (hi, decrement_tol) in [(inf, 0.0), (0.5, 0.0), (inf, 1e-30)] {
            let opts = LmOptions {
                decrement_tol,
                ..LmOptions::default()
            };
            let (lo, hi) = ([-inf, -inf], [hi, inf]);
            let whole = minimise(&Rosen, &[-1.2, 1.0], &lo, &hi, &opts).unwrap();
            assert!(whole.iterations > 4, "{whole:?}");
            let short = LmOptions {
                max_iterations: 4,
                ..opts
            };
            let (a, state) =
                minimise_resumable(&Rosen, &[-1.2, 1.0], &lo, &hi, &short, LmState::default())
                    .unwrap();
            assert_eq!(a.termination, Termination::MaxIterations);
            let rest = LmOptions {
                max_iterations: opts.max_iterations - a.iterations,
                ..opts
            };
            let (b, _) = minimise_resumable(&Rosen, &a.u, &lo, &hi, &rest, state).unwrap();
            assert_eq!(b.u, whole.u);
            assert_eq!(b.cost, whole.cost);
            assert_eq!(b.termination, whole.termination);
            assert_eq!(a.iterations + b.iterations, whole.iterations);
            assert_eq!(a.evaluations + b.evaluations, whole.evaluations + 1);
        }
    }

    #[test]
    fn cholesky_solves() {
        let a = [4.0, 2.0, 2.0, 3.0];
        let x = cholesky_solve(&a, &[2.0, 1.0], 2).unwrap();
        assert!((4.0 * x[0] + 2.0 * x[1] - 2.0).abs() < 1e-14);
        assert!((2.0 * x[0] + 3.0 * x[1] - 1.0).abs() < 1e-14);
        assert!(cholesky_solve(&[1.0, 2.0, 2.0, 1.0], &[1.0, 1.0], 2).is_none());
    }
}
