//! The virtual stepped-sine rig against exact steady states: the closed
//! form for a linear oscillator, exact first-order harmonic balance for the
//! weakly nonlinear wing (Tables 3 + 7), and the fold frequencies of a
//! strong Duffing oscillator.

mod support;
use nlsdof::excitation::Excitation;
use nlsdof::simulation::{simulate_excitation, Method, Options, State};
use nlsdof::stepped_sine::{run, run_levels, run_sweeps, RigOptions, RigSweep};
use nlsdof::{ForcedResponse, Formulation, Model, SweepDirection};
use std::f64::consts::{PI, TAU};
use support::fixtures::wing;

/// The paper's five input levels (Table 2, peak-to-peak) as zero-to-peak γ.
const LEVELS_PP: [f64; 5] = [0.82, 1.24, 1.62, 2.00, 2.46];

fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| a + (b - a) * k as f64 / (n - 1) as f64)
        .collect()
}

/// Linear oscillator: every rig point equals the closed-form steady state
/// `|X| = γ/|α − Ω² + iδΩ|`, `φ = arg(α − Ω² + iδΩ)`, in both sweep
/// directions, to 2e-4 in amplitude and 0.02° in phase; no step is
/// unsettled and the harmonics of a linear response vanish.
#[test]
fn linear_rig_settles_to_the_exact_steady_state() {
    let model = Model::linear(0.26699, 306.7878, 0.1164).unwrap();
    let m = model.normalised().unwrap();
    let omegas = linspace(TAU * 5.2, TAU * 5.6, 41);
    let gamma = 0.41;
    for dir in [SweepDirection::Up, SweepDirection::Down] {
        let sw = run(
            &m,
            gamma,
            &omegas,
            dir,
            &RigOptions::default(),
            State::default(),
        )
        .unwrap();
        assert_eq!(sw.points.len(), omegas.len());
        for p in &sw.points {
            let (re, im) = (m.alpha - p.omega * p.omega, m.delta * p.omega);
            let exact = gamma / re.hypot(im);
            let phase = im.atan2(re);
            let ea = (p.amplitude - exact).abs() / exact;
            let ep = (p.phase - phase).abs().to_degrees();
            assert!(p.settled, "{dir:?} f = {} Hz not settled", p.omega / TAU);
            assert!(
                ea < 2e-4 && ep < 0.02,
                "{dir:?} f = {:.4} Hz: amplitude error {ea:e}, phase error {ep}°",
                p.omega / TAU
            );
            assert!(p.harmonic2 < 1e-6 * exact && p.harmonic3 < 1e-6 * exact);
            assert!((p.peak_to_peak - 2.0 * exact).abs() < 1e-3 * exact);
            assert!((0.0..=PI).contains(&p.phase));
        }
    }
}

struct Cosine(f64, f64);
impl Excitation for Cosine {
    fn accel(&self, t: f64) -> f64 {
        self.0 * (self.1 * t).cos()
    }
}

/// Why the rig does not use the shaker's rule: from rest at resonance, the
/// first time two consecutive cycle amplitudes agree within 1 % the
/// response is still far from steady state (≈ 19 % error, asserted > 10 %:
/// the transient decays by only e^{−2πζ} ≈ 4 % per cycle), whereas the
/// rig's rule (geometric tail bound + minimum dwell) lands within 1e-4.
#[test]
fn naive_one_percent_rule_is_badly_wrong_for_light_damping() {
    let m = Model::linear(0.26699, 306.7878, 0.1164)
        .unwrap()
        .normalised()
        .unwrap();
    let w = (m.alpha - 0.5 * m.delta * m.delta).sqrt(); // amplitude resonance
    let gamma = 0.41;
    let exact = gamma / (m.alpha - w * w).hypot(m.delta * w);
    let n = 64;
    let cycles = 400;
    let mut xs = Vec::with_capacity(n * cycles + 1);
    simulate_excitation(
        &m,
        &Cosine(gamma, w),
        0.0,
        TAU / w / n as f64,
        n * cycles + 1,
        &Options {
            method: Method::Rk4 {
                samples_per_step: 1,
            },
            ..Default::default()
        },
        |s| xs.push(s.x),
    )
    .unwrap();
    let amp = |c: usize| {
        let (mut re, mut im) = (0.0, 0.0);
        for j in 0..n {
            let th = TAU * j as f64 / n as f64;
            re += xs[c * n + j] * th.cos();
            im += xs[c * n + j] * th.sin();
        }
        2.0 / n as f64 * re.hypot(im)
    };
    let naive = (1..cycles)
        .find(|&c| ((amp(c) - amp(c - 1)) / amp(c)).abs() < 0.01)
        .unwrap();
    let naive_err = (amp(naive) - exact).abs() / exact;
    println!("naive rule stops after {naive} cycles with error {naive_err:.3}");
    assert!(naive_err > 0.1, "naive rule error only {naive_err}");
    let sw = run(
        &m,
        gamma,
        &[w],
        SweepDirection::Up,
        &RigOptions::default(),
        State::default(),
    )
    .unwrap();
    let p = sw.points[0];
    let err = (p.amplitude - exact).abs() / exact;
    println!("rig: {} cycles, error {err:e}", p.cycles);
    assert!(
        p.settled && err < 1e-4,
        "rig error {err:e} after {} cycles",
        p.cycles
    );
}

fn hb_amplitude(model: &Model, gamma: f64, omega: f64, near: f64) -> f64 {
    let fr = ForcedResponse::new(model, gamma, Formulation::HarmonicBalance).unwrap();
    let rs = fr.steady_states(omega).unwrap();
    rs.roots
        .iter()
        .filter(|r| r.stable)
        .map(|r| r.amplitude)
        .min_by(|a, b| (a - near).abs().total_cmp(&(b - near).abs()))
        .expect("a stable steady state")
}

/// Weak nonlinearity (wing, Table 3 + Table 7, real exponents ρ = 4.0022,
/// η = 3.03099): the paper's test — five levels (Table 2), 200 steps of
/// 1 mHz from 5.3 Hz, sweep up — every settled amplitude agrees with the
/// exact first-order harmonic-balance amplitude within 0.5 % and the phase
/// within 0.5°.
#[test]
fn wing_rig_matches_harmonic_balance_within_half_percent() {
    let model = wing();
    let m = model.normalised().unwrap();
    let omegas: Vec<f64> = (0..200).map(|k| TAU * (5.3 + 0.001 * k as f64)).collect();
    let gammas: Vec<f64> = LEVELS_PP.iter().map(|pp| 0.5 * pp).collect();
    let sweeps: Vec<RigSweep> = run_levels(
        &m,
        &gammas,
        &omegas,
        SweepDirection::Up,
        &RigOptions::default(),
        &|| {},
    )
    .unwrap();
    let mut worst = (0.0f64, 0.0f64);
    for sw in &sweeps {
        let fr = ForcedResponse::new(&model, sw.gamma, Formulation::HarmonicBalance).unwrap();
        for p in &sw.points {
            assert!(
                p.settled,
                "γ = {} f = {} Hz not settled",
                sw.gamma,
                p.omega / TAU
            );
            let rs = fr.steady_states(p.omega).unwrap();
            assert_eq!(rs.roots.len(), 1, "the wing has a single steady state");
            let hb = rs.roots[0];
            let ea = (p.amplitude - hb.amplitude).abs() / hb.amplitude;
            let ep = (p.phase - hb.phase).abs().to_degrees();
            worst = (worst.0.max(ea), worst.1.max(ep));
            assert!(
                ea < 0.005,
                "γ = {} f = {:.4} Hz: rig {} vs HB {} ({ea:e})",
                sw.gamma,
                p.omega / TAU,
                p.amplitude,
                hb.amplitude
            );
            assert!(
                ep < 0.5,
                "γ = {} f = {:.4} Hz: phase {} vs HB {}",
                sw.gamma,
                p.omega / TAU,
                p.phase,
                hb.phase
            );
        }
    }
    let cycles: usize = sweeps
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.cycles))
        .sum();
    println!(
        "wing rig vs HB: worst amplitude error {:.3e}, phase {:.3}°, {cycles} cycles",
        worst.0, worst.1
    );
}

/// Strong Duffing (ζ = 1 %, β a²/α ≈ 0.4 at the peak, resonance shifted
/// ~14 %): sweeping up, the rig follows the resonant branch and drops at
/// the upper fold; sweeping down it follows the low branch and jumps up at
/// the lower fold — each within one frequency step of the harmonic-balance
/// fold, and away from the jump within 2 % of the HB amplitude of the
/// branch being followed.
#[test]
fn strong_duffing_rig_jumps_at_the_fold_within_one_step() {
    let model = Model::linear(1.0, 1.0, 0.02)
        .unwrap()
        .with_stiffness(0.5, 2.0)
        .unwrap();
    let m = model.normalised().unwrap();
    let gamma = 0.02;
    let omegas = linspace(0.9, 1.3, 161);
    let step = omegas[1] - omegas[0];
    let fr = ForcedResponse::new(&model, gamma, Formulation::HarmonicBalance).unwrap();
    let folds = fr.folds(0.9, 1.3).unwrap();
    assert_eq!(folds.len(), 2, "expected two folds, got {folds:?}");
    let (lower, upper) = (folds[0].omega, folds[1].omega);
    let opts = RigOptions::default();
    for dir in [SweepDirection::Up, SweepDirection::Down] {
        let sw = run(&m, gamma, &omegas, dir, &opts, State::default()).unwrap();
        let pts = &sw.points;
        // the jump: largest amplitude ratio between consecutive steps
        let (k, ratio) = (0..pts.len() - 1)
            .map(|k| (k, (pts[k + 1].amplitude / pts[k].amplitude).ln().abs()))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        let (w0, w1) = (pts[k].omega, pts[k + 1].omega);
        let fold = if dir == SweepDirection::Up {
            upper
        } else {
            lower
        };
        println!(
            "{dir:?}: jump between {w0:.5} and {w1:.5} rad/s (amplitude ×{:.2}), HB fold {fold:.5}, step {step:.5}",
            ratio.exp()
        );
        assert!(
            ratio > 1.5f64.ln(),
            "no jump found (largest ratio {})",
            ratio.exp()
        );
        let (lo, hi) = (w0.min(w1), w0.max(w1));
        assert!(
            lo - step <= fold && fold <= hi + step,
            "{dir:?}: jump [{lo}, {hi}] vs fold {fold}"
        );
        // branch followed: compare to the HB root nearest the rig amplitude,
        // away from the jump (two steps) where slow settling is legitimate
        for (i, p) in pts.iter().enumerate() {
            if i + 2 >= k && i <= k + 3 {
                continue;
            }
            let hb = hb_amplitude(&model, gamma, p.omega, p.amplitude);
            let e = (p.amplitude - hb).abs() / hb;
            assert!(
                e < 0.02,
                "{dir:?} ω = {}: rig {} vs HB {} ({e:e})",
                p.omega,
                p.amplitude,
                hb
            );
        }
    }
}

/// The rig's parallel runs are bit-identical on 1 and 2 threads and equal
/// to running each sweep alone, in the documented order.
#[test]
fn parallel_sweeps_are_identical_on_any_number_of_threads() {
    let m = wing().normalised().unwrap();
    let omegas: Vec<f64> = (0..12).map(|k| TAU * (5.3 + 0.02 * k as f64)).collect();
    let gammas = [0.41, 0.81, 1.23];
    let dirs = [SweepDirection::Up, SweepDirection::Down];
    let opts = RigOptions::default();
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| run_sweeps(&m, &gammas, &omegas, &dirs, &opts, &|| {}).unwrap())
    };
    let (one, two) = (on(1), on(2));
    assert_eq!(one, two);
    for (d, &dir) in dirs.iter().enumerate() {
        for (k, &g) in gammas.iter().enumerate() {
            let alone = run(&m, g, &omegas, dir, &opts, Default::default()).unwrap();
            assert_eq!(one[d * gammas.len() + k], alone);
        }
    }
    let levels = run_levels(&m, &gammas, &omegas, SweepDirection::Down, &opts, &|| {}).unwrap();
    assert_eq!(levels[..], one[gammas.len()..]);
}

/// The rig's Richardson estimate of its integration error against the true
/// error of a linear oscillator (closed-form steady state), stepped at a
/// quarter and at a sixth of its natural frequency with 16 samples per input
/// cycle, where RK4 resolves the input but not the structure: the estimate is
/// within a factor 2 of the true error, which is above 1e-3 (warned). (Measured:
/// 3.67e-3 for 3.36e-3 at f_n/4, and 2.76e-3 for 1.84e-3 at f_n/6, where
/// ω_n h = 2.36 is far from the asymptotic regime of the h⁴ law.)
/// At the default 64 samples per cycle near resonance both are small.
#[test]
fn integration_error_estimate_matches_the_true_error() {
    let (wn, zeta) = (TAU * 10.0, 0.02);
    let m = Model::linear(1.0, wn * wn, 2.0 * zeta * wn)
        .unwrap()
        .normalised()
        .unwrap();
    let exact = |w: f64| 1.0 / ((m.alpha - w * w).hypot(m.delta * w));
    let coarse = RigOptions {
        samples_per_cycle: 16,
        ..RigOptions::default()
    };
    for f in [2.5, 10.0 / 6.0] {
        let sw = run(
            &m,
            1.0,
            &[TAU * f],
            SweepDirection::Up,
            &coarse,
            State::default(),
        )
        .unwrap();
        let p = sw.points[0];
        let truth = (p.amplitude - exact(p.omega)).abs() / exact(p.omega);
        assert!(truth > 1e-3, "f = {f}: true error {truth:e}");
        let ratio = p.integration_error / truth;
        assert!(
            (0.5..=2.0).contains(&ratio),
            "f = {f}: estimate {:e}, true error {truth:e}",
            p.integration_error
        );
    }
    let sw = run(
        &m,
        1.0,
        &linspace(TAU * 9.5, TAU * 10.5, 5),
        SweepDirection::Up,
        &RigOptions::default(),
        State::default(),
    )
    .unwrap();
    for p in &sw.points {
        let truth = (p.amplitude - exact(p.omega)).abs() / exact(p.omega);
        assert!(
            p.integration_error < 1e-4 && truth < 1e-4,
            "{p:?}, true error {truth:e}"
        );
    }
}
