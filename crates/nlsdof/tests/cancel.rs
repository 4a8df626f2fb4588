//! Cooperative cancellation (issue 27, item 5): a cancelled identification,
//! fit, landscape, profile or time-domain fit returns its typed
//! *interrupted* error and nothing partial; a flag that is never set
//! changes no result.

mod support;

use nlsdof::cancel::{Cancel, Interrupted};
use nlsdof::harmonic_balance::SweepDirection;
use nlsdof::identification::profile::{
    output_error_profile, output_error_profile_with, ProfileError,
};
use nlsdof::identification::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use support::fixtures::hb_sweeps as data;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// One test at a time: the tests share rayon's pool, and a thread of a
/// cancelled run that waits in a join can pick up a long task of another
/// test's (uncancelled) fit, which would be measured as its latency.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn serial() -> std::sync::MutexGuard<'static, ()> {
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

/// Duffing + quadratic damping with jumps, 3 levels, up and down.
fn duffing_quadratic_data() -> Dataset {
    let wn = TWO_PI * 10.0;
    let t = Parameters::from([wn * wn, 2.0 * 0.01 * wn, 4.0e6, 2.0, 0.05, 1.0, 1.0]);
    data(
        &t,
        &[0.5, 1.0, 2.0],
        (8.0, 14.0),
        60,
        &[SweepDirection::Up, SweepDirection::Down],
        None,
    )
}

#[test]
fn a_cancelled_identify_returns_the_interrupted_error() {
    let _one_at_a_time = serial();
    static SET: AtomicBool = AtomicBool::new(true);
    let d = duffing_quadratic_data();
    let mut plan = FitPlan::new(ModelKind::Generalised);
    plan.lm.cancel = Cancel::new(&SET);
    let r = identify(&d, &plan, &|_| {});
    assert!(
        matches!(r, Err(IdentifyError::Interrupted(Interrupted))),
        "{r:?}"
    );
}

/// The flag set mid-run — by the progress callback, as the candidates'
/// race (the output-error stage) of a long multistart identification
/// begins, so that the run is certainly under way whatever the machine's
/// speed (a flag set after a fixed 0.2 s from another thread missed the
/// run once its exact data stopped escalating) — stops it within a fraction
/// of a second, with the error.
#[test]
fn identify_stops_soon_after_the_flag_is_set_mid_run() {
    let _one_at_a_time = serial();
    static STOP: AtomicBool = AtomicBool::new(false);
    let d = duffing_quadratic_data();
    let mut plan = FitPlan::new(ModelKind::Generalised);
    plan.starts = 4000;
    plan.lm.cancel = Cancel::new(&STOP);
    let set_at = std::sync::Mutex::new(None);
    let r = identify(&d, &plan, &|e| {
        if let IdentifyProgress::Stage { name, .. } = e {
            let mut at = set_at.lock().unwrap();
            if name.starts_with("output error") && at.is_none() {
                *at = Some(Instant::now());
                STOP.store(true, Ordering::Relaxed);
            }
        }
    });
    let ended = Instant::now();
    let at = set_at
        .lock()
        .unwrap()
        .expect("the race (output-error stage) began");
    let latency = ended.duration_since(at);
    eprintln!("identify stopped {latency:?} after the flag");
    assert!(
        matches!(r, Err(IdentifyError::Interrupted(_))),
        "{:?}",
        r.map(|id| id.fit.theta)
    );
    assert!(latency < Duration::from_millis(500), "{latency:?}");
}

#[test]
fn a_flag_never_set_changes_nothing_and_a_set_one_stops_fit_and_profile() {
    let _one_at_a_time = serial();
    static CLEAR: AtomicBool = AtomicBool::new(false);
    static SET: AtomicBool = AtomicBool::new(true);
    let d = duffing_quadratic_data();
    let spec = FitSpec::new(ModelKind::DuffingGeneralised, &d);
    let plain = FitOptions {
        starts: 6,
        ..FitOptions::default()
    };
    let mut flagged = plain.clone();
    flagged.lm.cancel = Cancel::new(&CLEAR);
    let a = fit(&d, &spec, &plain, &|| {}).unwrap();
    let b = fit(&d, &spec, &flagged, &|| {}).unwrap();
    assert_eq!(a, b);
    let mut stopped = plain.clone();
    stopped.lm.cancel = Cancel::new(&SET);
    assert!(matches!(
        fit(&d, &spec, &stopped, &|| {}),
        Err(FitError::Interrupted(Interrupted))
    ));
    // the profile: bit for bit without a set flag, the error with one
    let p = Parameter::Eta;
    let step = nlsdof::identification::profile::default_step(&a, p);
    let plain = output_error_profile(&d, &spec, &a.theta, p, step, 3).unwrap();
    let calls = std::sync::atomic::AtomicUsize::new(0);
    let flagged = output_error_profile_with(
        &d,
        &spec,
        &a.theta,
        p,
        step,
        3,
        Cancel::new(&CLEAR),
        &|done, most| {
            assert!(done <= most && most == 7);
            calls.fetch_add(1, Ordering::Relaxed);
        },
    )
    .unwrap();
    assert_eq!(plain, flagged);
    assert_eq!(calls.load(Ordering::Relaxed), plain.fits);
    assert!(matches!(
        output_error_profile_with(
            &d,
            &spec,
            &a.theta,
            p,
            step,
            3,
            Cancel::new(&SET),
            &|_, _| {}
        ),
        Err(ProfileError::Interrupted(_)) | Err(ProfileError::Fit(FitError::Interrupted(_)))
    ));
}
